// link_engine: serves request frames on the register bus and streams telemetry.
//
// Requests (from frame_rx): READ_REQ -> one bus read -> READ_RESP or ERROR; WRITE_REQ -> one bus
// write -> WRITE_ACK or ERROR; SNAPSHOT_REQ -> bus reads of SNAP_SEQ (which latches the snapshot),
// SNAP_TIMESTAMP, SNAP_COUNT0..3, SNAP_DIR and SNAP_STATUS -> SNAPSHOT_RESP, one consistent window.
// Parser errors (bad CRC, malformed) are answered with ERROR frames. A bus error is classified with
// the generated map: unknown address -> BAD_ADDRESS, write to a read-only register -> READ_ONLY,
// otherwise the register refused the value -> BAD_VALUE; the detail byte is the address.
// Streaming: with stream_en_i, each captured window (win_valid_i) is sent as one TELEMETRY frame
// as soon as the transmitter is free, between responses, and acknowledged with win_consumed_o.
// Every body field is placed at its offset in the generated layout (OMNILOC_BODY_*_LSB / _W of
// common/regmap.json "frames.layouts"); frame_tx reads body byte k (bits [8k+7:8k]) through
// tx_idx_i / tx_byte_o while it sends, so the body is held, and no request or window is taken,
// until frame_tx is idle again (tx_ready_i).
// Assumptions: the register bus acks every access within a bounded time (encoder_regs: 1 cycle).
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module link_engine #(
    parameter integer BODY_BYTES = `OMNILOC_FRAME_TELEMETRY_BODY_BYTES,
    parameter integer IDX_W = $clog2(BODY_BYTES + 1)
) (
    input  wire                    clk_i,
    input  wire                    rst_i,
    // events from frame_rx
    input  wire                    ev_valid_i,
    output wire                    ev_ready_o,
    input  wire                    ev_error_i,
    input  wire [7:0]              ev_code_i,
    input  wire [`OMNILOC_ADDR_W-1:0] ev_addr_i,
    input  wire [`OMNILOC_DATA_W-1:0] ev_data_i,
    // frames to frame_tx
    output reg                     tx_start_o,
    input  wire                    tx_ready_i,
    output reg  [7:0]              tx_type_o,
    output reg  [7:0]              tx_body_len_o,
    input  wire [IDX_W-1:0]        tx_idx_i,
    output wire [7:0]              tx_byte_o,
    // register bus master
    output reg  [`OMNILOC_ADDR_W-1:0] reg_addr_o,
    output reg                     reg_rd_o,
    output reg                     reg_wr_o,
    output reg  [`OMNILOC_DATA_W-1:0] reg_wdata_o,
    input  wire [`OMNILOC_DATA_W-1:0] reg_rdata_i,
    input  wire                    reg_ack_i,
    input  wire                    reg_err_i,
    // window stream from the core
    input  wire                    stream_en_i,
    input  wire                    win_valid_i,
    input  wire [`OMNILOC_DATA_W-1:0] win_seq_i,
    input  wire [`OMNILOC_DATA_W-1:0] win_timestamp_i,
    input  wire [`OMNILOC_CHANNELS*`OMNILOC_DATA_W-1:0] win_count_i,
    input  wire [`OMNILOC_CHANNELS-1:0] win_dir_i,
    input  wire [`OMNILOC_BODY_WINDOW_STATUS_W-1:0] status_i,
    output reg                     win_consumed_o
);

    localparam integer ADDR_W   = `OMNILOC_ADDR_W;
    localparam integer DATA_W   = `OMNILOC_DATA_W;
    localparam integer CH       = `OMNILOC_CHANNELS;
    localparam integer STATUS_W = `OMNILOC_BODY_WINDOW_STATUS_W;   // the status byte of a window

    localparam [2:0] S_IDLE = 3'd0, S_BUS = 3'd1, S_SEND = 3'd2, S_SNAP = 3'd3;

    reg [2:0]  state_q;
    reg        tele_pending_q;
    reg [7:0]        req_code_q;
    reg [ADDR_W-1:0] req_addr_q;
    reg [2:0]        snap_step_q;
    reg [8*BODY_BYTES-1:0] body_q;

    // Body byte tx_idx_i (an index past the body reads as 0).
    wire [8*BODY_BYTES+7:0] body_ext = {8'd0, body_q};
    localparam [IDX_W-1:0] LAST_IDX = BODY_BYTES[IDX_W-1:0];
    assign tx_byte_o = (tx_idx_i < LAST_IDX) ? body_ext[8*tx_idx_i +: 8] : 8'd0;
    // frame_tx has or is sending the body: registered (a cycle late when it ends, never when it
    // starts, since tx_start_o itself counts), so that no ready depends on tx_ready_i in the same cycle.
    reg  tx_busy_q;
    wire tx_busy = tx_start_o || tx_busy_q;

    // Field slots of the body layouts.
    localparam integer W_SEQ   = `OMNILOC_BODY_WINDOW_SEQ_LSB;
    localparam integer W_TS    = `OMNILOC_BODY_WINDOW_TIMESTAMP_CYCLES_LSB;
    localparam integer W_COUNT = `OMNILOC_BODY_WINDOW_COUNT_LSB;
    localparam integer W_DIR   = `OMNILOC_BODY_WINDOW_DIR_LSB;
    localparam integer W_STAT  = `OMNILOC_BODY_WINDOW_STATUS_LSB;
    localparam integer DIR_W   = `OMNILOC_BODY_WINDOW_DIR_W;

    // A TELEMETRY body from the window bank (dir zero-extended to its byte).
    function [8*BODY_BYTES-1:0] window_body(input [DATA_W-1:0] seq, input [DATA_W-1:0] ts,
                                            input [CH*DATA_W-1:0] count, input [CH-1:0] dir,
                                            input [STATUS_W-1:0] stat);
        begin
            window_body = {8*BODY_BYTES{1'b0}};
            window_body[W_SEQ +: `OMNILOC_BODY_WINDOW_SEQ_W] = seq;
            window_body[W_TS +: `OMNILOC_BODY_WINDOW_TIMESTAMP_CYCLES_W] = ts;
            window_body[W_COUNT +: `OMNILOC_BODY_WINDOW_COUNT_N * `OMNILOC_BODY_WINDOW_COUNT_W] = count;
            window_body[W_DIR +: DIR_W] = {{(DIR_W - CH){1'b0}}, dir};
            window_body[W_STAT +: `OMNILOC_BODY_WINDOW_STATUS_W] = stat;
        end
    endfunction

    // tx_start_o is a valid held until frame_tx takes the frame (tx_ready_i); the body stays stable.
    assign ev_ready_o = (state_q == S_IDLE) && !tx_busy && !tele_pending_q;

    // Snapshot read order; the body slot of each read follows the SNAPSHOT_RESP layout.
    function [ADDR_W-1:0] snap_addr(input [2:0] step);
        case (step)
            3'd0:    snap_addr = `OMNILOC_REG_SNAP_SEQ;
            3'd1:    snap_addr = `OMNILOC_REG_SNAP_TIMESTAMP;
            3'd2:    snap_addr = `OMNILOC_REG_SNAP_COUNT0;
            3'd3:    snap_addr = `OMNILOC_REG_SNAP_COUNT1;
            3'd4:    snap_addr = `OMNILOC_REG_SNAP_COUNT2;
            3'd5:    snap_addr = `OMNILOC_REG_SNAP_COUNT3;
            3'd6:    snap_addr = `OMNILOC_REG_SNAP_DIR;
            default: snap_addr = `OMNILOC_REG_SNAP_STATUS;   // STATUS as it stood at that capture
        endcase
    endfunction

    wire [7:0] bus_err_code = !(`OMNILOC_ADDR_KNOWN(req_addr_q)) ? `OMNILOC_ERR_BAD_ADDRESS :
                              (req_code_q == `OMNILOC_FRAME_WRITE_REQ && !(`OMNILOC_ADDR_WRITABLE(req_addr_q)))
                                  ? `OMNILOC_ERR_READ_ONLY : `OMNILOC_ERR_BAD_VALUE;

    task send(input [7:0] frame_type, input [7:0] body_len);
        begin
            tx_type_o     <= frame_type;
            tx_body_len_o <= body_len;
            state_q       <= S_SEND;
        end
    endtask

    always @(posedge clk_i) begin
        if (rst_i) begin
            state_q        <= S_IDLE;
            tele_pending_q <= 1'b0;
            tx_busy_q      <= 1'b1;
            req_code_q     <= 8'd0;
            req_addr_q     <= {ADDR_W{1'b0}};
            snap_step_q    <= 3'd0;
            tx_start_o     <= 1'b0;
            tx_type_o      <= 8'd0;
            tx_body_len_o  <= 8'd0;
            reg_addr_o     <= {ADDR_W{1'b0}};
            reg_rd_o       <= 1'b0;
            reg_wr_o       <= 1'b0;
            reg_wdata_o    <= {DATA_W{1'b0}};
            win_consumed_o <= 1'b0;
        end else begin
            if (tx_start_o && tx_ready_i) tx_start_o <= 1'b0;
            tx_busy_q      <= tx_start_o || !tx_ready_i;
            reg_rd_o       <= 1'b0;
            reg_wr_o       <= 1'b0;
            win_consumed_o <= 1'b0;
            if (win_valid_i && stream_en_i) tele_pending_q <= 1'b1;

            case (state_q)
                S_IDLE: begin
                    if (tx_busy) begin
                        // wait until frame_tx has sent the previous frame
                    end else if (tele_pending_q && !win_valid_i) begin
                        // Telemetry goes first: it is the time-critical traffic.
                        tele_pending_q <= 1'b0;
                        win_consumed_o <= 1'b1;
                        tx_type_o      <= `OMNILOC_FRAME_TELEMETRY;
                        tx_body_len_o  <= `OMNILOC_FRAME_TELEMETRY_BODY_BYTES;
                        body_q      <= window_body(win_seq_i, win_timestamp_i, win_count_i, win_dir_i, status_i);
                        tx_start_o     <= 1'b1;
                    end else if (ev_valid_i) begin
                        req_code_q <= ev_code_i;
                        req_addr_q <= ev_addr_i;
                        body_q  <= {8*BODY_BYTES{1'b0}};
                        if (ev_error_i) begin
                            body_q[`OMNILOC_BODY_ERROR_CODE_LSB +: `OMNILOC_BODY_ERROR_CODE_W] <= ev_code_i;
                            body_q[`OMNILOC_BODY_ERROR_DETAIL_LSB +: `OMNILOC_BODY_ERROR_DETAIL_W] <= ev_addr_i;
                            send(`OMNILOC_FRAME_ERROR, `OMNILOC_FRAME_ERROR_BODY_BYTES);
                        end else if (ev_code_i == `OMNILOC_FRAME_SNAPSHOT_REQ) begin
                            snap_step_q <= 3'd0;
                            reg_addr_o  <= snap_addr(3'd0);
                            reg_rd_o    <= 1'b1;
                            state_q     <= S_SNAP;
                        end else begin
                            reg_addr_o  <= ev_addr_i;
                            reg_wdata_o <= ev_data_i;
                            reg_rd_o    <= (ev_code_i == `OMNILOC_FRAME_READ_REQ);
                            reg_wr_o    <= (ev_code_i == `OMNILOC_FRAME_WRITE_REQ);
                            state_q     <= S_BUS;
                        end
                    end
                end
                S_BUS: if (reg_ack_i) begin
                    if (reg_err_i) begin
                        body_q[`OMNILOC_BODY_ERROR_CODE_LSB +: `OMNILOC_BODY_ERROR_CODE_W] <= bus_err_code;
                        body_q[`OMNILOC_BODY_ERROR_DETAIL_LSB +: `OMNILOC_BODY_ERROR_DETAIL_W] <= req_addr_q;
                        send(`OMNILOC_FRAME_ERROR, `OMNILOC_FRAME_ERROR_BODY_BYTES);
                    end else if (req_code_q == `OMNILOC_FRAME_READ_REQ) begin
                        body_q[`OMNILOC_BODY_REG_VALUE_ADDR_LSB +: `OMNILOC_BODY_REG_VALUE_ADDR_W] <= req_addr_q;
                        body_q[`OMNILOC_BODY_REG_VALUE_DATA_LSB +: `OMNILOC_BODY_REG_VALUE_DATA_W] <= reg_rdata_i;
                        send(`OMNILOC_FRAME_READ_RESP, `OMNILOC_FRAME_READ_RESP_BODY_BYTES);
                    end else begin
                        body_q[`OMNILOC_BODY_REG_ADDR_ADDR_LSB +: `OMNILOC_BODY_REG_ADDR_ADDR_W] <= req_addr_q;
                        send(`OMNILOC_FRAME_WRITE_ACK, `OMNILOC_FRAME_WRITE_ACK_BODY_BYTES);
                    end
                end
                S_SNAP: if (reg_ack_i) begin
                    // Each read goes to its field of the WINDOW layout (same order as snap_addr).
                    case (snap_step_q)
                        3'd0:    body_q[W_SEQ +: `OMNILOC_BODY_WINDOW_SEQ_W] <= reg_rdata_i;
                        3'd1:    body_q[W_TS +: `OMNILOC_BODY_WINDOW_TIMESTAMP_CYCLES_W] <= reg_rdata_i;
                        3'd2:    body_q[W_COUNT + 0 * `OMNILOC_BODY_WINDOW_COUNT_W +: `OMNILOC_BODY_WINDOW_COUNT_W] <= reg_rdata_i;
                        3'd3:    body_q[W_COUNT + 1 * `OMNILOC_BODY_WINDOW_COUNT_W +: `OMNILOC_BODY_WINDOW_COUNT_W] <= reg_rdata_i;
                        3'd4:    body_q[W_COUNT + 2 * `OMNILOC_BODY_WINDOW_COUNT_W +: `OMNILOC_BODY_WINDOW_COUNT_W] <= reg_rdata_i;
                        3'd5:    body_q[W_COUNT + 3 * `OMNILOC_BODY_WINDOW_COUNT_W +: `OMNILOC_BODY_WINDOW_COUNT_W] <= reg_rdata_i;
                        3'd6:    body_q[W_DIR +: DIR_W] <= reg_rdata_i[DIR_W-1:0];
                        default: body_q[W_STAT +: `OMNILOC_BODY_WINDOW_STATUS_W] <= reg_rdata_i[`OMNILOC_BODY_WINDOW_STATUS_W-1:0];
                    endcase
                    if (snap_step_q == 3'd7) begin
                        send(`OMNILOC_FRAME_SNAPSHOT_RESP, `OMNILOC_FRAME_SNAPSHOT_RESP_BODY_BYTES);
                    end else begin
                        snap_step_q <= snap_step_q + 3'd1;
                        reg_addr_o  <= snap_addr(snap_step_q + 3'd1);
                        reg_rd_o    <= 1'b1;
                    end
                end
                default: if (!tx_start_o) begin   // S_SEND
                    tx_start_o <= 1'b1;
                    state_q    <= S_IDLE;
                end
            endcase
        end
    end

endmodule

`default_nettype wire
