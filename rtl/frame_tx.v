// frame_tx: serialises one frame (SYNC, LEN, TYPE, body, CRC-16 high byte first) into bytes.
//
// The body is not copied: frame_tx reads it byte by byte from its source, body_idx_o (a register)
// naming the byte it wants and body_byte_i carrying it in the same cycle; the byte is registered
// the cycle after the index moves and only then put out. The caller holds the body (and type_i,
// body_len_i are taken at start) until ready_o is high again.
// Assumptions: body_len_i <= MAX_BODY_BYTES. Guarantees: LEN = body_len + 1; the CRC covers LEN,
// TYPE and body; one frame at a time, bytes in order, none dropped.
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module frame_tx #(
    parameter integer MAX_BODY_BYTES = `OMNILOC_FRAME_TELEMETRY_BODY_BYTES,
    parameter integer IDX_W = $clog2(MAX_BODY_BYTES + 1)
) (
    input  wire                        clk_i,
    input  wire                        rst_i,
    input  wire                        start_i,
    output wire                        ready_o,
    input  wire [7:0]                  type_i,
    input  wire [7:0]                  body_len_i,
    output wire [IDX_W-1:0]            body_idx_o,  // the body byte wanted
    input  wire [7:0]                  body_byte_i, // body byte body_idx_o, combinational
    output reg  [7:0]                  byte_o,
    output reg                         byte_valid_o,
    input  wire                        byte_ready_i
);

localparam [2:0] S_IDLE = 3'd0, S_LEN = 3'd1, S_TYPE = 3'd2, S_BODY = 3'd3,
                 S_CRC_HI = 3'd4, S_CRC_LO = 3'd5, S_SYNC = 3'd6;

reg [2:0]                  state_q;
reg [7:0]                  type_q;
reg [7:0]                  len_q;
reg [7:0]                  left_q;
reg [IDX_W-1:0]            idx_q;
reg [7:0]                  body_byte_q;   // body byte idx_q, valid when body_ok_q
reg                        body_ok_q;
reg [15:0]                 crc_q;

assign ready_o = (state_q == S_IDLE);
assign body_idx_o = idx_q;

// The byte that goes out next, by state, and the CRC after it.
reg [7:0] next_byte;
always @(*) begin
    case (state_q)
        S_SYNC:   next_byte = `OMNILOC_FRAME_SYNC;
        S_LEN:    next_byte = len_q;
        S_TYPE:   next_byte = type_q;
        S_BODY:   next_byte = body_byte_q;
        S_CRC_HI: next_byte = crc_q[15:8];
        default:  next_byte = crc_q[7:0];
    endcase
end
wire [15:0] crc_next;
crc16_ccitt crc_step (.crc_i(crc_q), .data_i(next_byte), .crc_o(crc_next));

// The output register can take a byte (a body byte only once it has been fetched).
wire slot_free = (!byte_valid_o || byte_ready_i) && (state_q != S_BODY || body_ok_q);
wire advance = (state_q == S_BODY) && slot_free;

// Data registers: no reset (each is written before it is used).
always @(posedge clk_i) begin
    body_byte_q <= body_byte_i;
    if (state_q == S_IDLE) begin
        type_q <= type_i;
        len_q  <= body_len_i + 8'd1;
    end
    if (slot_free) byte_o <= next_byte;
end

always @(posedge clk_i) begin
    if (rst_i) begin
        state_q      <= S_IDLE;
        left_q       <= 8'd0;
        idx_q        <= {IDX_W{1'b0}};
        body_ok_q    <= 1'b0;
        crc_q        <= `OMNILOC_CRC_INIT;
        byte_valid_o <= 1'b0;
    end else begin
        body_ok_q <= !advance;
        if (byte_valid_o && byte_ready_i) byte_valid_o <= 1'b0;
        if (state_q == S_IDLE) begin
            idx_q <= {IDX_W{1'b0}};
            if (start_i) begin
                left_q  <= body_len_i;
                crc_q   <= `OMNILOC_CRC_INIT;
                state_q <= S_SYNC;
            end
        end else if (slot_free) begin
            byte_valid_o <= 1'b1;
            case (state_q)
                S_SYNC: state_q <= S_LEN;
                S_LEN: begin
                    crc_q   <= crc_next;
                    state_q <= S_TYPE;
                end
                S_TYPE: begin
                    crc_q   <= crc_next;
                    state_q <= (left_q == 8'd0) ? S_CRC_HI : S_BODY;
                end
                S_BODY: begin
                    crc_q   <= crc_next;
                    idx_q   <= idx_q + 1'b1;
                    left_q  <= left_q - 8'd1;
                    if (left_q == 8'd1) state_q <= S_CRC_HI;
                end
                S_CRC_HI: state_q <= S_CRC_LO;
                default:  state_q <= S_IDLE;   // S_CRC_LO
            endcase
        end
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
always @(*) if (!f_past_valid) assume(rst_i);   // start from reset
always @(*) assume(body_len_i <= MAX_BODY_BYTES);
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i)) begin
        // A byte on offer is held until the UART takes it.
        if ($past(byte_valid_o) && !$past(byte_ready_i)) assert(byte_valid_o && byte_o == $past(byte_o));
        // A frame starts with SYNC: after it is put out, LEN is next.
        if (state_q == S_LEN) assert(byte_valid_o && byte_o == `OMNILOC_FRAME_SYNC || !byte_valid_o);
        if (state_q == S_LEN) assert(byte_o == `OMNILOC_FRAME_SYNC);
        if (state_q == S_BODY) assert(left_q != 8'd0);
        assert(left_q <= MAX_BODY_BYTES);
    end
end

// Each property reachable: a frame with a body of two bytes sent to its last CRC byte.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (state_q == S_IDLE && $past(state_q) == S_CRC_LO && len_q == 8'd3);
    end
end
`endif

endmodule

`default_nettype wire
