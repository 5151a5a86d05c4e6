// link_engine: serves request frames on the register bus and streams telemetry.
//
// Requests (from frame_rx): READ_REQ -> one bus read -> READ_RESP or ERROR; WRITE_REQ -> one bus
// write -> WRITE_ACK or ERROR; SNAPSHOT_REQ -> one bus read of SNAP_SEQ (which latches the frozen
// window bank of encoder_regs) -> SNAPSHOT_RESP, its body the bank read byte by byte.
// Parser errors (bad CRC, malformed) are answered with ERROR frames. A bus error is classified with
// the generated map: unknown address -> BAD_ADDRESS, write to a read-only register -> READ_ONLY,
// otherwise the register refused the value -> BAD_VALUE; the detail byte is the address.
// Streaming: with stream_en_i, each captured window (win_valid_i) is sent as one TELEMETRY frame
// as soon as the transmitter is free, between responses: win_consumed_o latches the frozen bank
// and acknowledges the window, and the frame's body is the bank.
// Every body field is placed at its offset in the generated layout (OMNILOC_BODY_*_LSB / _W of
// common/regmap.json "frames.layouts"); frame_tx reads body byte k (bits [8k+7:8k]) through
// tx_idx_i / tx_byte_o while it sends, so the body is held, and no request or window is taken,
// until frame_tx is idle again (tx_ready_i).
// The bus answer (ack, error, data) is registered before the FSM decides on it; decisions are
// registered (state_q, small_q, tx_*), so no bus or frame_tx output feeds a wide enable directly.
// Assumptions: the register bus acks every access within a bounded time (encoder_regs: 3 cycles, pipelined).
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
    input  wire                    ev_read_i,    // frame_rx's decoded kind: READ_REQ / WRITE_REQ,
    input  wire                    ev_write_i,   // neither = SNAPSHOT_REQ (both 0 with ev_error_i)
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
    // window stream from the core: the frozen bank is latched by win_consumed_o (and by a read of
    // SNAP_SEQ) and read byte by byte (bank_byte_i is byte tx_idx_i of it)
    input  wire                    stream_en_i,
    input  wire                    win_valid_i,
    input  wire [7:0]              bank_byte_i,
    output reg                     win_consumed_o
);

localparam integer ADDR_W   = `OMNILOC_ADDR_W;
localparam integer DATA_W   = `OMNILOC_DATA_W;
localparam integer SMALL_BYTES = `OMNILOC_BODY_REG_VALUE_BYTES;   // the largest non-window body

localparam [1:0] S_IDLE = 2'd0, S_BUS = 2'd1, S_SEND = 2'd2, S_SNAP = 2'd3;

reg [1:0]  state_q;
reg        tele_pending_q;
reg [7:0]        req_code_q;
reg [ADDR_W-1:0] req_addr_q;
// The body: the frozen bank (TELEMETRY, SNAPSHOT_RESP) or the small body of the other answers.
reg                     from_bank_q;
reg [8*SMALL_BYTES-1:0] small_q;
// The bus answer, registered before any decision is taken on it (pipelined bus).
reg              ack_q, err_q;
reg [DATA_W-1:0] rdata_q;

// Body byte tx_idx_i (an index past the small body reads as 0).
localparam [IDX_W-1:0] SMALL_IDX = SMALL_BYTES[IDX_W-1:0];
wire [8*SMALL_BYTES+7:0] small_ext = {8'd0, small_q};
wire [7:0] small_byte = (tx_idx_i < SMALL_IDX) ? small_ext[8*tx_idx_i +: 8] : 8'd0;
assign tx_byte_o = from_bank_q ? bank_byte_i : small_byte;

// frame_tx has or is sending the body: registered (a cycle late when it ends, never when it
// starts, since tx_start_o itself counts), so that no ready depends on tx_ready_i in the same cycle.
reg  tx_busy_q;
wire tx_busy = tx_start_o || tx_busy_q;

// tx_start_o is a valid held until frame_tx takes the frame (tx_ready_i); the body stays stable.
assign ev_ready_o = (state_q == S_IDLE) && !tx_busy && !tele_pending_q;

wire [7:0] bus_err_code = !(`OMNILOC_ADDR_KNOWN(req_addr_q)) ? `OMNILOC_ERR_BAD_ADDRESS :
                          (req_code_q == `OMNILOC_FRAME_WRITE_REQ && !(`OMNILOC_ADDR_WRITABLE(req_addr_q)))
                              ? `OMNILOC_ERR_READ_ONLY : `OMNILOC_ERR_BAD_VALUE;

// Data registers: no reset (each is written before the frame that sends it starts).
always @(posedge clk_i) begin
    rdata_q <= reg_rdata_i;
    err_q   <= reg_err_i;
end

always @(posedge clk_i) begin
    if (rst_i) begin
        state_q        <= S_IDLE;
        tele_pending_q <= 1'b0;
        tx_busy_q      <= 1'b1;
        ack_q          <= 1'b0;
        from_bank_q    <= 1'b0;
        tx_start_o     <= 1'b0;
        reg_rd_o       <= 1'b0;
        reg_wr_o       <= 1'b0;
        win_consumed_o <= 1'b0;
    end else begin
        if (tx_start_o && tx_ready_i) tx_start_o <= 1'b0;
        tx_busy_q      <= tx_start_o || !tx_ready_i;
        ack_q          <= reg_ack_i;
        reg_rd_o       <= 1'b0;
        reg_wr_o       <= 1'b0;
        win_consumed_o <= 1'b0;
        // A window captured just before the bank was frozen for telemetry is the one frozen
        // (win_consumed_o latches the bank at this edge): it is not sent twice.
        if (win_valid_i && stream_en_i && !win_consumed_o) tele_pending_q <= 1'b1;

        case (state_q)
            S_IDLE: begin
                if (tx_busy) begin
                    // wait until frame_tx has sent the previous frame
                end else if (tele_pending_q && !win_valid_i) begin
                    // Telemetry goes first: it is the time-critical traffic.
                    tele_pending_q <= 1'b0;
                    win_consumed_o <= 1'b1;
                    from_bank_q    <= 1'b1;
                    tx_type_o      <= `OMNILOC_FRAME_TELEMETRY;
                    tx_body_len_o  <= `OMNILOC_FRAME_TELEMETRY_BODY_BYTES;
                    tx_start_o     <= 1'b1;
                end else if (ev_valid_i) begin
                    req_code_q  <= ev_code_i;
                    req_addr_q  <= ev_addr_i;
                    from_bank_q <= 1'b0;
                    small_q     <= {8*SMALL_BYTES{1'b0}};
                    if (ev_error_i) begin
                        small_q[`OMNILOC_BODY_ERROR_CODE_LSB +: `OMNILOC_BODY_ERROR_CODE_W] <= ev_code_i;
                        small_q[`OMNILOC_BODY_ERROR_DETAIL_LSB +: `OMNILOC_BODY_ERROR_DETAIL_W] <= ev_addr_i;
                        tx_type_o     <= `OMNILOC_FRAME_ERROR;
                        tx_body_len_o <= `OMNILOC_FRAME_ERROR_BODY_BYTES;
                        state_q       <= S_SEND;
                    end else if (!ev_read_i && !ev_write_i) begin   // SNAPSHOT_REQ
                        // Reading SNAP_SEQ latches the frozen bank: the answer is the bank.
                        reg_addr_o <= `OMNILOC_REG_SNAP_SEQ;
                        reg_rd_o   <= 1'b1;
                        state_q    <= S_SNAP;
                    end else begin
                        reg_addr_o  <= ev_addr_i;
                        reg_wdata_o <= ev_data_i;
                        reg_rd_o    <= ev_read_i;
                        reg_wr_o    <= ev_write_i;
                        state_q     <= S_BUS;
                    end
                end
            end
            S_BUS: if (ack_q) begin
                if (err_q) begin
                    small_q[`OMNILOC_BODY_ERROR_CODE_LSB +: `OMNILOC_BODY_ERROR_CODE_W] <= bus_err_code;
                    small_q[`OMNILOC_BODY_ERROR_DETAIL_LSB +: `OMNILOC_BODY_ERROR_DETAIL_W] <= req_addr_q;
                    tx_type_o     <= `OMNILOC_FRAME_ERROR;
                    tx_body_len_o <= `OMNILOC_FRAME_ERROR_BODY_BYTES;
                end else if (req_code_q == `OMNILOC_FRAME_READ_REQ) begin
                    small_q[`OMNILOC_BODY_REG_VALUE_ADDR_LSB +: `OMNILOC_BODY_REG_VALUE_ADDR_W] <= req_addr_q;
                    small_q[`OMNILOC_BODY_REG_VALUE_DATA_LSB +: `OMNILOC_BODY_REG_VALUE_DATA_W] <= rdata_q;
                    tx_type_o     <= `OMNILOC_FRAME_READ_RESP;
                    tx_body_len_o <= `OMNILOC_FRAME_READ_RESP_BODY_BYTES;
                end else begin
                    small_q[`OMNILOC_BODY_REG_ADDR_ADDR_LSB +: `OMNILOC_BODY_REG_ADDR_ADDR_W] <= req_addr_q;
                    tx_type_o     <= `OMNILOC_FRAME_WRITE_ACK;
                    tx_body_len_o <= `OMNILOC_FRAME_WRITE_ACK_BODY_BYTES;
                end
                state_q <= S_SEND;
            end
            S_SNAP: if (ack_q) begin
                from_bank_q   <= 1'b1;
                tx_type_o     <= `OMNILOC_FRAME_SNAPSHOT_RESP;
                tx_body_len_o <= `OMNILOC_FRAME_SNAPSHOT_RESP_BODY_BYTES;
                state_q       <= S_SEND;
            end
            default: begin   // S_SEND: the body and type are registered; start the frame
                tx_start_o <= 1'b1;
                state_q    <= S_IDLE;
            end
        endcase
    end
end

endmodule

`default_nettype wire
